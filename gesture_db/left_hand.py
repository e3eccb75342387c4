"""The left hand as a gesture: describe a note's pitch contour, and play a description back.

A recording's left-hand contour is ``pitch_deviation_cents`` (cents from the nominal pitch of
the note being played, :data:`data_schemas.recording.RECORDING`). A vibrato is an
oscillation, which a few Bezier segments cannot follow; so each note's contour is turned
into a slowly varying *description* that they can (:func:`describe_left_hand`), laid out as
:data:`LEFT_HAND_LAYOUT` (:data:`LEFT_HAND_DIM` numbers):

- ``intonation`` (cents): the median of the contour's centre line (below);
- ``onset_delay`` (s): when the vibrato starts (the first zero crossing of a kept
  half-cycle; the note's duration when it has none);
- ``glide_time`` (s): the span at the note's end where the finger already slides to the
  next note (a shift's portamento), 0 without one;
- ``extent`` (cents, peak): the vibrato extent envelope from the onset to the note's end,
  2 cubic Bezier segments (:func:`gesture_db.bezier.fit_segments`, 9 numbers);
- ``rate`` (Hz): the vibrato rate envelope over the same span, 1 cubic Bezier segment
  (5 numbers).

The extraction method: (1) the glide is the trailing run of frames more than
:data:`GLIDE_CENTS` from the median of the note's first 80 %; the rest is the body; (2) the
body is smoothed by a 25 ms moving average (sensor noise; the peaks are divided by its gain
at the note's rate); (3) a first centre line is its moving average over one period of a
:data:`DEFAULT_RATE` vibrato, whose zero crossings give a first rate; the centre line is
then the moving average over one period of that rate (which cancels a sine of that rate);
(4) the oscillation (body minus centre) is cut at its zero crossings into half-cycles; those
whose peak reaches :data:`MIN_EXTENT` cents are the vibrato (the longest stretch of
consecutive ones, less a first or last one under :data:`RELATIVE_EXTENT` of its neighbour's
peak, where the centre line bends): their peaks, at their middles, give the extent envelope
(held before the first and after the last), and each pair of half-cycles (one cycle) gives a
rate at its middle (the first and last cycles left out); a short vibrato (fewer than
:data:`SHORT_CROSSINGS` zero crossings) is instead one sine with a linear extent fitted by
least squares (:func:`sine_fit`); the envelopes are sampled on the frames from the onset to
the end and fitted with Bezier segments. A note with fewer than :data:`MIN_HALF_CYCLES` kept
half-cycles has no vibrato (extent 0, rate :data:`DEFAULT_RATE`, onset delay = its
duration).

:func:`left_hand_cents` plays a description back over a target note of another duration:
the onset delay is kept in seconds (scaled down on a shorter note), the envelopes are
stretched over the rest, and the vibrato is re-synthesised as ``intonation + extent(t)
sin(phase(t))`` with ``phase`` the integral of the rate, continued from the previous note.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from gesture_db.bezier import evaluate_segments, fit_segments

#: Names and lengths of the parts of a left-hand description, in order.
LEFT_HAND_LAYOUT = (("intonation", 1), ("onset_delay", 1), ("glide_time", 1), ("extent", 9),
                    ("rate", 5))
#: Length of a left-hand description.
LEFT_HAND_DIM = sum(n for _name, n in LEFT_HAND_LAYOUT)
#: Bezier segments of the extent and rate envelopes.
EXTENT_SEGMENTS = 2
RATE_SEGMENTS = 1
#: Rate (Hz) assumed for the first centre line and given to notes without vibrato.
DEFAULT_RATE = 5.5
#: A half-cycle whose peak (cents) reaches this is vibrato.
MIN_EXTENT = 2.0
#: ... and, first or last, this share of the peak of the half-cycle beside it.
RELATIVE_EXTENT = 0.5
#: A note needs this many vibrato half-cycles to have a vibrato.
MIN_HALF_CYCLES = 2
#: A vibrato with fewer zero crossings than this is short: one sine is fitted to it.
SHORT_CROSSINGS = 7
#: Frames this far (cents) from the note's median at its end are a glide to the next note.
GLIDE_CENTS = 45.0
#: Rates (Hz) a vibrato may have.
RATE_RANGE = (3.0, 9.0)
_SMOOTH = 0.025  # s, moving average against sensor noise
_DENSE = 256  # points an envelope is evaluated on before interpolation


def _slices() -> dict[str, slice]:
    out, k = {}, 0
    for name, n in LEFT_HAND_LAYOUT:
        out[name] = slice(k, k + n)
        k += n
    return out


#: Where each part of :data:`LEFT_HAND_LAYOUT` sits in a description.
PARTS = _slices()


def left_hand_value_mask() -> np.ndarray:
    """Which entries of a description are values (not Bezier shares or handle ratios).

    Examples
    --------
    >>> left_hand_value_mask().astype(int).tolist()
    [1, 1, 1, 0, 0, 1, 1, 1, 0, 0, 0, 0, 0, 1, 1, 0, 0]
    """
    def bezier(n: int) -> list[bool]:
        return [False] * n + [True] * (n + 1) + [False] * (2 * n)

    return np.array([True, True, True] + bezier(EXTENT_SEGMENTS) + bezier(RATE_SEGMENTS),
                    bool)


def moving_average(x: np.ndarray, width: int) -> np.ndarray:
    """Centred moving average over ``width`` frames, the window shrinking at the ends.

    Examples
    --------
    >>> moving_average(np.array([0.0, 3.0, 0.0, 3.0]), 3).tolist()
    [1.5, 1.0, 2.0, 1.5]
    """
    x = np.asarray(x, np.float64)
    width = int(max(width, 1))
    if width == 1 or x.size == 0:
        return x.copy()
    c = np.r_[0.0, np.cumsum(x)]
    i = np.arange(x.size)
    lo = np.clip(i - width // 2, 0, x.size)
    hi = np.clip(i - width // 2 + width, 0, x.size)
    return (c[hi] - c[lo]) / (hi - lo)


def _zero_crossings(y: np.ndarray) -> np.ndarray:
    """Sub-frame indices where ``y`` changes sign."""
    s = np.signbit(y)
    k = np.flatnonzero(s[1:] != s[:-1])
    return k + y[k] / (y[k] - y[k + 1])


def _half_cycles(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start, end (sub-frame indices) and peak |y| of each half-cycle between zero crossings."""
    z = _zero_crossings(y)
    if z.size < 2:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    a, b = z[:-1], z[1:]
    # the frames strictly between two crossings; each half-cycle holds at least one
    cuts = np.floor(z).astype(np.int64) + 1  # first frame after each crossing (< y.size)
    peaks = np.maximum.reduceat(np.abs(y), cuts)[: a.size]
    return a, b, peaks


def _vibrato_cycles(body: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                         np.ndarray]:
    """Centre line and the kept half-cycles (start, end, peak) of a glide-free body."""
    xs = moving_average(body, round(_SMOOTH * fs))
    centre = moving_average(xs, round(fs / DEFAULT_RATE))
    a, b, peak = _half_cycles(xs - centre)
    keep = peak >= MIN_EXTENT
    if keep.sum() >= MIN_HALF_CYCLES:
        rate0 = float(np.clip(0.5 * fs / np.median(b[keep] - a[keep]), *RATE_RANGE))
        centre = moving_average(xs, round(fs / rate0))
        a, b, peak = _half_cycles(xs - centre)
        keep = peak >= MIN_EXTENT
    # keep the longest stretch of consecutive kept half-cycles
    runs = np.split(np.flatnonzero(keep), np.flatnonzero(np.diff(np.flatnonzero(keep)) > 1)
                    + 1) if keep.any() else []
    best = list(max(runs, key=len)) if runs else []
    # the centre line bends where a vibrato starts or stops: a bump much smaller than the
    # half-cycle beside it is not one
    while len(best) > 1 and peak[best[0]] < RELATIVE_EXTENT * peak[best[1]]:
        best.pop(0)
    while len(best) > 1 and peak[best[-1]] < RELATIVE_EXTENT * peak[best[-2]]:
        best.pop()
    best = np.asarray(best, np.int64)
    return centre, a[best], b[best], peak[best]


def describe_left_hand(cents: np.ndarray, frame_rate: float) -> np.ndarray:
    """The left-hand description of one note's pitch contour (see the module docstring).

    Parameters
    ----------
    cents : np.ndarray [shape=(n,)], cents
        The note's ``pitch_deviation_cents`` frames from its onset to its offset.
    frame_rate : float, Hz
        Frames per second.

    Returns
    -------
    np.ndarray [shape=(LEFT_HAND_DIM,)]

    Examples
    --------
    >>> fs = 240.0
    >>> t = np.arange(0, 1.0, 1 / fs)
    >>> x = 5.0 + np.where(t >= 0.2, 12.0 * np.sin(2 * np.pi * 6.0 * (t - 0.2)), 0.0)
    >>> d = describe_left_hand(x, fs)
    >>> round(float(d[0])), round(float(d[1]), 1), round(float(mean_extent(d)))
    (5, 0.2, 12)
    >>> round(float(mean_rate(d)), 1)
    6.0
    """
    x = np.asarray(cents, np.float64)
    if frame_rate <= 0 or x.ndim != 1 or not np.isfinite(x).all():
        raise ParameterError("describe_left_hand needs a finite 1-D contour and a rate > 0")
    n = x.size
    fs = float(frame_rate)
    duration = max(n - 1, 1) / fs
    if n < 4:
        return _description(float(np.median(x)) if n else 0.0, duration, 0.0,
                            np.zeros(2), np.full(2, DEFAULT_RATE))
    ref = float(np.median(x[:max(int(0.8 * n), 1)]))
    far = np.abs(x - ref) > GLIDE_CENTS
    k = n
    while k > 0 and far[k - 1] and (n - k) < 0.2 * fs:
        k -= 1
    glide = (n - k) / fs if n - k >= 2 and k > n // 2 else 0.0
    body = x[:k] if glide > 0 else x
    centre, a, b, peak = _vibrato_cycles(body, fs)
    intonation = float(np.median(centre))
    if a.size < MIN_HALF_CYCLES:
        return _description(intonation, duration, glide, np.zeros(n),
                            np.full(n, DEFAULT_RATE))
    grid = np.arange(int(np.ceil(a[0])), n, dtype=np.float64)
    if grid.size < 2:
        grid = np.array([n - 2.0, n - 1.0])
    mid = 0.5 * (a + b)
    extent = np.interp(grid, mid, peak)
    z = np.r_[a, b[-1]]
    if z.size < SHORT_CROSSINGS:  # a short vibrato: one sine fitted to it
        rate_hz, extent = sine_fit(body[int(np.ceil(a[0])):], fs)
        extent = np.interp(grid - grid[0], np.arange(extent.size), extent)
        return _description(intonation, a[0] / fs, glide, extent,
                            np.full(grid.size, rate_hz))
    z = z[1:-1]  # the first and last cycles lean on the bent ends of the centre line
    rates = fs / (z[2:] - z[:-2])
    rate = np.interp(grid, 0.5 * (z[2:] + z[:-2]), np.clip(rates, *RATE_RANGE))
    # undo the smoothing's attenuation of a sine at the note's rate
    arg = np.pi * float(np.median(rate)) * max(round(_SMOOTH * fs), 1) / fs
    extent = extent * (arg / np.sin(arg))
    return _description(intonation, a[0] / fs, glide, extent, rate)


def sine_fit(x: np.ndarray, fs: float) -> tuple[float, np.ndarray]:
    """Rate (Hz) and extent envelope (cents, per frame) of a short vibrato by least squares.

    Fits ``p0 + p1 t + (a0 + a1 t) sin(2 pi f t) + (b0 + b1 t) cos(2 pi f t)`` on a grid
    of rates ``f`` (:data:`RATE_RANGE`, 0.1 Hz steps, then 0.01 Hz around the best); a span
    shorter than two cycles of :data:`DEFAULT_RATE` fits ``p0 + a0 sin + b0 cos`` only
    (the slopes would trade off against a slow sine). The extent never exceeds 1.25 times
    the span's largest deviation from its median.

    Examples
    --------
    >>> t = np.arange(0, 0.3, 1 / 240)
    >>> rate, extent = sine_fit(3 + 10 * np.sin(2 * np.pi * 5.7 * t + 1), 240.0)
    >>> round(rate, 2), round(float(extent.mean()), 1)
    (5.7, 10.0)
    """
    x = np.asarray(x, np.float64)
    t = np.arange(x.size) / fs
    tc = t - t.mean() if t.size else t

    def fit(freqs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual sums of squares and coefficients per rate (normal equations, batched)."""
        w = 2 * np.pi * freqs[:, None] * t[None, :]
        s, c = np.sin(w), np.cos(w)
        one = np.ones_like(s)
        parts = [one, one * tc, s, tc * s, c, tc * c] if linear else [one, s, c]
        basis = np.stack(parts, axis=2)  # (F, n, 6 or 3)
        gram = np.matmul(basis.transpose(0, 2, 1), basis) + 1e-9 * np.eye(len(parts))
        rhs = basis.transpose(0, 2, 1) @ x
        coef = np.linalg.solve(gram, rhs[..., None])[..., 0]
        return float(x @ x) - np.einsum("fi,fi->f", coef, rhs), coef

    if x.size < 8:
        return DEFAULT_RATE, np.zeros(max(x.size, 2))
    linear = x.size / fs >= 2.0 / DEFAULT_RATE
    coarse = np.arange(RATE_RANGE[0], RATE_RANGE[1] + 1e-9, 0.1)
    best = coarse[int(np.argmin(fit(coarse)[0]))]
    fine = np.clip(np.arange(best - 0.1, best + 0.1 + 1e-9, 0.01), *RATE_RANGE)
    sse, coefs = fit(fine)
    k = int(np.argmin(sse))
    rate, coef = float(fine[k]), coefs[k]
    if linear:
        extent = np.hypot(coef[2] + coef[3] * tc, coef[4] + coef[5] * tc)
    else:
        extent = np.full(x.size, float(np.hypot(coef[1], coef[2])))
    return rate, np.minimum(extent, 1.25 * float(np.max(np.abs(x - np.median(x)))))


def _description(intonation: float, delay: float, glide: float, extent: np.ndarray,
                 rate: np.ndarray) -> np.ndarray:
    """Pack the parts, fitting the envelopes (frames of the note) with Bezier segments."""
    free2 = np.zeros((EXTENT_SEGMENTS, 2), np.int64)
    free1 = np.zeros((RATE_SEGMENTS, 2), np.int64)
    ext, _ = fit_segments(np.maximum(extent, 0.0), free2, max_candidates=16)
    rat, _ = fit_segments(rate, free1, max_candidates=16)
    return np.r_[intonation, delay, glide, ext, rat]


def _envelope(vector: np.ndarray, n_segments: int, x: np.ndarray) -> np.ndarray:
    """A Bezier envelope at positions ``x`` in [0, 1] of its note."""
    dense = evaluate_segments(vector, n_segments, _DENSE)
    return np.interp(np.clip(x, 0.0, 1.0), np.linspace(0.0, 1.0, _DENSE), dense)


def mean_extent(description: np.ndarray) -> float:
    """Mean peak extent (cents) of a description's vibrato after its onset (0 without)."""
    d = np.asarray(description, np.float64)
    return float(np.maximum(evaluate_segments(d[PARTS["extent"]], EXTENT_SEGMENTS, _DENSE),
                            0.0).mean())


def mean_rate(description: np.ndarray) -> float:
    """Mean rate (Hz) of a description's rate envelope."""
    d = np.asarray(description, np.float64)
    return float(evaluate_segments(d[PARTS["rate"]], RATE_SEGMENTS, _DENSE).mean())


def left_hand_cents(description: np.ndarray, sample_duration: float, target_duration: float,
                    t: np.ndarray, *, phase: float = 0.0,
                    vibrato: bool = True) -> tuple[np.ndarray, float]:
    """Play a left-hand description back over a target note.

    Parameters
    ----------
    description : np.ndarray [shape=(LEFT_HAND_DIM,)]
        From :func:`describe_left_hand`, of a sample note of ``sample_duration`` s.
    sample_duration, target_duration : float, s
        Durations of the sample and of the target note (> 0).
    t : np.ndarray [shape=(m,)], s
        Times from the target's onset (increasing).
    phase : float, rad
        Vibrato phase at the target's onset (the previous note's end phase: continuous).
    vibrato : bool
        False plays the intonation only (a trilled note, say).

    Returns
    -------
    cents : np.ndarray [shape=(m,)], cents
        Pitch deviation from the target's nominal pitch.
    end_phase : float, rad
        The phase at ``target_duration`` (for the next note).

    Examples
    --------
    >>> d = np.r_[4.0, 0.0, 0.0, [0.5, 0.5, 10, 10, 10, 1/3, 2/3, 1/3, 2/3],
    ...           [1.0, 5.0, 5.0, 1/3, 2/3]]
    >>> c, end = left_hand_cents(d, 1.0, 2.0, np.array([0.0, 0.05]), phase=np.pi / 2)
    >>> c.round(3).tolist(), round(end % (2 * np.pi), 3)
    ([14.0, 4.0], 1.571)
    """
    d = np.asarray(description, np.float64)
    ds, dt = float(sample_duration), float(target_duration)
    if d.shape != (LEFT_HAND_DIM,) or not (ds > 0 and dt > 0):
        raise ParameterError(f"a left-hand description has {LEFT_HAND_DIM} numbers and "
                             f"positive durations (got {d.shape}, {ds}, {dt})")
    t = np.asarray(t, np.float64)
    intonation = float(d[PARTS["intonation"]][0])
    delay_s = float(np.clip(d[PARTS["onset_delay"]][0], 0.0, ds))
    delay_t = delay_s * min(1.0, dt / ds)
    # target time -> sample time: the delay kept, the rest stretched
    tt = np.clip(t, 0.0, dt)
    u = np.where(tt < delay_t, tt * (delay_s / delay_t if delay_t > 0 else 1.0),
                 delay_s + (tt - delay_t) * (ds - delay_s) / max(dt - delay_t, 1e-9))
    x = (u - delay_s) / max(ds - delay_s, 1e-9)
    rate = _envelope(d[PARTS["rate"]], RATE_SEGMENTS, x)
    extent = np.where(tt >= delay_t, np.maximum(_envelope(d[PARTS["extent"]],
                                                          EXTENT_SEGMENTS, x), 0.0), 0.0)
    rate = np.clip(rate, *RATE_RANGE)
    steps = np.diff(t, prepend=t[0] if t.size else 0.0)
    ph = phase + 2.0 * np.pi * np.cumsum(rate * steps)
    cents = intonation + (extent * np.sin(ph) if vibrato else 0.0)
    last = float(ph[-1]) if t.size else phase
    if t.size:
        tail = max(dt - float(t[-1]), 0.0)
        last += 2.0 * np.pi * float(rate[-1]) * tail
    return np.asarray(cents, np.float64), last


def stopped_notes(notes: pd.DataFrame) -> np.ndarray:
    """Which database notes were stopped by a finger (not played on an open string)."""
    from data_schemas.instruments import instrument_facts

    out = np.zeros(len(notes), bool)
    inst = (notes["instrument"].fillna("violin").astype(str).to_numpy() if "instrument" in notes
            else np.full(len(notes), "violin"))
    for name in np.unique(inst):
        rows = inst == name
        opens = instrument_facts(str(name)).open_pitch(notes["string"].to_numpy(int)[rows])
        out[rows] = notes["midi_pitch"].to_numpy(int)[rows] != opens
    return out


def _present(vec) -> bool:
    return vec is not None and not (isinstance(vec, float) and np.isnan(vec))


class LeftHandSource:
    """The left hands of database notes, to be played on stopped target notes.

    A stopped sample gives its own description; a sample played on an open string (whose
    left hand did nothing, for want of a finger) gives its group's mean left hand (the
    centre of the group's left-hand Gaussian, fitted on its stopped notes); a note without
    a description, or a database of schema 1.0 / 1.1, gives None.

    Parameters
    ----------
    db : gesture_db.store.GestureDB
    """

    def __init__(self, db) -> None:
        self.db = db
        self._by_id: dict[str, np.ndarray] | None = None

    def _load(self) -> dict[str, np.ndarray]:
        notes = self.db.notes()
        out: dict[str, np.ndarray] = {}
        if "left_hand" not in notes:
            return out
        from gesture_db.store import left_hand_model_from_row

        models = {}
        for _, row in self.db.models().iterrows():
            model = left_hand_model_from_row(row)
            if model is not None:
                models[row["group"]] = model
        stopped = stopped_notes(notes)
        for nid, group, vec, own in zip(notes["note_id"], notes["group"], notes["left_hand"],
                                        stopped, strict=True):
            if not _present(vec):
                continue
            if own:
                out[str(nid)] = np.asarray(vec, np.float64)
            elif group in models:
                out[str(nid)] = models[group].param_mean
        return out

    def get(self, note_id: str) -> np.ndarray | None:
        """The left hand of ``note_id`` (shape ``(LEFT_HAND_DIM,)``), None without one."""
        if self._by_id is None:
            self._by_id = self._load()
        return self._by_id.get(str(note_id))

    @property
    def n_described(self) -> int:
        """Notes with a left-hand description."""
        if self._by_id is None:
            self._by_id = self._load()
        return len(self._by_id)


def describe_notes(cents: np.ndarray, bounds: pd.DataFrame | np.ndarray,
                   frame_rate: float) -> list[list[float] | None]:
    """Descriptions of several notes of one take (None where its contour has nulls).

    Parameters
    ----------
    cents : np.ndarray [shape=(n,)], cents
        The take's ``pitch_deviation_cents`` (NaN where null).
    bounds : np.ndarray [shape=(k, 2)], int
        First and last frame of each note.
    frame_rate : float, Hz
    """
    out: list[list[float] | None] = []
    for a, b in np.asarray(bounds, np.int64):
        seg = cents[int(a):int(b) + 1]
        out.append(None if seg.size == 0 or not np.isfinite(seg).all()
                   else describe_left_hand(seg, frame_rate).tolist())
    return out


__all__ = ["DEFAULT_RATE", "LEFT_HAND_DIM", "LEFT_HAND_LAYOUT", "LeftHandSource", "PARTS",
           "stopped_notes",
           "describe_left_hand", "describe_notes", "left_hand_cents", "left_hand_value_mask",
           "mean_extent", "mean_rate", "moving_average", "sine_fit"]
