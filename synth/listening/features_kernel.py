"""One hop of the streaming features as numba kernels (over plain arrays only).

:class:`synth.listening.features.StreamingFeatures` allocates the buffers and tables once
and calls :func:`push_hop` per hop; the slow numpy twins that check these kernels live in
``tests/naive_features.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from synth.listening.feature_spec import (
    AMIN,
    COL_APERIODICITY,
    COL_CENTROID,
    COL_CREST,
    COL_FLATNESS,
    COL_FLUX,
    COL_PITCH_DIFF,
    COL_RMS_DB,
    COL_ROLLOFF,
    COL_ZCR,
    PITCH_CLIP,
    RMS_FLOOR,
    ROLL_PERCENT,
    YIN_THRESHOLD,
)
from synth.listening.fft_kernel import irfft, rfft

#: Rows of :func:`push_hop`'s ``work`` array [shape=(WORK_ROWS, yin_window + 2)]: the YIN
#: buffer's spectrum (real, imaginary), its first half's spectrum, complex FFT scratch, the
#: frame's magnitude, YIN's cross-correlation (with the next row: the windowed frame's
#: spectrum when the YIN buffer is longer than a frame), the energy, the CMND and the
#: windowed frame.
(WORK_X_RE, WORK_X_IM, WORK_H_RE, WORK_H_IM, WORK_Z_RE, WORK_Z_IM, WORK_MAGNITUDE,
 WORK_CROSS, WORK_ENERGY, WORK_CMND, WORK_FRAME) = range(11)
WORK_ROWS = 11


@njit(cache=True)
def push_hop(buf, hop, expected_f0, sample_rate, has_previous, window, freqs, norm, work,
             halves, slot, use_ring, rev, tables, frame_rev, frame_tables,
             out):  # pragma: no cover - numba
    """One hop of ``StreamingFeatures``: shift ``hop`` into ``buf``, features into ``out``.

    ``window`` is the frame's Hann window, ``freqs`` its bins' frequencies (Hz), ``norm``
    the previous frame's normalised magnitude (updated), ``halves`` [shape=(n, 2, w/2 + 1)]
    the kept spectra of the buffer's newest halves; ``rev, tables`` and ``frame_rev,
    frame_tables`` are :func:`synth.listening.fft_kernel.rfft_tables` of the buffer's length
    and of the frame's.

    The buffer's spectrum is that of its zero-padded halves, ``X[f] = A[f] + (-1)**f B[f]``;
    ``B`` (the newest half) is computed and kept in ``halves[slot]``, which held the spectrum
    of the half that has since become the first one when ``use_ring`` (every push since was
    one hop and the half is a whole number of hops), else ``A`` is computed too.

    ``work`` rows: ``WORK_*``. Writes the columns of ``out`` up to ``aperiodicity``
    (``pitch_fine`` and ``rms_slope`` derive from them outside).
    """
    w = buf.size
    k = hop.size
    if k >= w:
        for i in range(w):
            buf[i] = hop[k - w + i]
    else:
        for i in range(w - k):
            buf[i] = buf[i + k]
        for i in range(k):
            buf[w - k + i] = hop[i]
    n_frame = window.size
    m = w // 2
    half = n_frame // 2
    x_re = work[WORK_X_RE]
    x_im = work[WORK_X_IM]
    h_re = work[WORK_H_RE]
    h_im = work[WORK_H_IM]
    zr = work[WORK_Z_RE, :m]
    zi = work[WORK_Z_IM, :m]
    mag = work[WORK_MAGNITUDE, :half + 1]
    pitched = np.isfinite(expected_f0) and expected_f0 > 0.0
    silent = True
    if pitched:
        for i in range(w):
            if buf[i] != 0.0:
                silent = False
                break
    p_re = halves[slot, 0]
    p_im = halves[slot, 1]
    need_x = w == n_frame or (pitched and not silent)
    if need_x:
        if use_ring:
            for i in range(m + 1):
                h_re[i] = p_re[i]
                h_im[i] = p_im[i]
        else:
            rfft(buf, m, h_re, h_im, zr, zi, rev, tables)
    rfft(buf[m:], m, p_re, p_im, zr, zi, rev, tables)
    if need_x:
        for i in range(0, m + 1, 2):
            x_re[i] = h_re[i] + p_re[i]
            x_im[i] = h_im[i] + p_im[i]
        for i in range(1, m + 1, 2):
            x_re[i] = h_re[i] - p_re[i]
            x_im[i] = h_im[i] - p_im[i]
    if w == n_frame:
        for i in range(half + 1):
            lo = i - 1 if i > 0 else 1
            hi = i + 1 if i < half else half - 1
            s_lo = -1.0 if i == 0 else 1.0
            s_hi = -1.0 if i == half else 1.0
            re = 0.5 * x_re[i] - 0.25 * (x_re[lo] + x_re[hi])
            im = 0.5 * x_im[i] - 0.25 * (s_lo * x_im[lo] + s_hi * x_im[hi])
            mag[i] = np.sqrt(re * re + im * im)
    else:
        frame = work[WORK_FRAME, :n_frame]
        for i in range(n_frame):
            frame[i] = buf[w - n_frame + i] * window[i]
        f_re = work[WORK_CROSS, :half + 1]
        f_im = work[WORK_ENERGY, :half + 1]
        rfft(frame, n_frame, f_re, f_im, work[WORK_Z_RE, :half], work[WORK_Z_IM, :half],
             frame_rev, frame_tables)
        for i in range(half + 1):
            mag[i] = np.sqrt(f_re[i] * f_re[i] + f_im[i] * f_im[i])
    spectral_features(buf[w - n_frame:], mag, freqs, norm, has_previous, out)
    if not pitched or silent:
        out[COL_PITCH_DIFF] = 0.0
        out[COL_APERIODICITY] = 1.0
        return
    for i in range(m + 1):
        # X conj(A)
        a = x_re[i] * h_re[i] + x_im[i] * h_im[i]
        b = x_im[i] * h_re[i] - x_re[i] * h_im[i]
        h_re[i] = a
        h_im[i] = b
    cross = work[WORK_CROSS, :w]
    irfft(h_re, h_im, cross, zr, zi, rev, tables)
    pitch, aper = yin_pitch(buf, cross, expected_f0, sample_rate, work[WORK_ENERGY, :w + 1],
                            work[WORK_CMND, :m + 1])
    diff = 0.0
    if np.isfinite(pitch) and pitch > 0.0:
        diff = 12.0 * np.log2(pitch / expected_f0)
    out[COL_PITCH_DIFF] = min(max(diff, -PITCH_CLIP), PITCH_CLIP)
    out[COL_APERIODICITY] = aper


@njit(cache=True)
def spectral_features(frame, mag, freqs, norm, has_previous, out):  # pragma: no cover - numba
    """Spectral and time-domain features of one frame (see ``features.frame_features``).

    ``frame`` is the frame's audio, ``mag`` its windowed magnitude spectrum and ``freqs``
    the bins' frequencies (Hz). Writes zcr, centroid, rolloff, flux, crest, flatness and
    rms_db into their columns of ``out`` and replaces ``norm`` (the previous frame's
    L2-normalised magnitude) by this frame's.
    """
    n = mag.size
    total = 0.0
    weighted = 0.0
    sq = 0.0
    peak = 0.0
    log_power = 0.0
    power_sum = 0.0
    product = 1.0
    for i in range(n):
        m = mag[i]
        total += m
        weighted += m * freqs[i]
        sq += m * m
        if m > peak:
            peak = m
        p = max(m * m, AMIN)
        # One log per product of 16 powers instead of 16 logs: each power is in
        # [1e-10, 2.7e5] for audio within +-1 (|X| <= sum of the window = 512), so the
        # product neither under- nor overflows (up to audio of ~1e6).
        product *= p
        if i % 16 == 15:
            log_power += np.log(product)
            product = 1.0
        power_sum += p
    log_power += np.log(product)
    centroid = weighted / total if total > 0 else 0.0
    threshold = ROLL_PERCENT * total
    cum = 0.0
    idx = 0
    for i in range(n):
        cum += mag[i]
        if cum >= threshold:
            idx = i
            break
    length = max(np.sqrt(sq), AMIN)
    flux = 0.0
    for i in range(n):
        v = mag[i] / length
        if has_previous:
            flux += (v - norm[i]) ** 2
        norm[i] = v
    w = frame.size
    crossings = 0
    energy = 0.0
    prev_neg = False
    for i in range(w):
        x = frame[i]
        energy += x * x
        neg = x < 0.0 and abs(x) > AMIN
        if i and neg != prev_neg:
            crossings += 1
        prev_neg = neg
    out[COL_ZCR] = crossings / w
    out[COL_CENTROID] = centroid
    out[COL_ROLLOFF] = freqs[idx]
    out[COL_FLUX] = np.sqrt(flux)
    out[COL_CREST] = peak / max(total / n, AMIN)
    out[COL_FLATNESS] = np.exp(log_power / n) / (power_sum / n)
    out[COL_RMS_DB] = 20.0 * np.log10(max(np.sqrt(energy / w), RMS_FLOOR))


@njit(cache=True)
def yin_pitch(x, cross, expected_f0, sample_rate, energy, cmnd):  # pragma: no cover - numba
    """YIN pitch (Hz) and aperiodicity of one frame from its FFT cross-correlation.

    ``cross[tau]`` is sum_j x[j] x[j + tau] over the frame's first half (lags 0 .. w/2);
    ``energy`` [shape=(w + 1,)] and ``cmnd`` [shape=(w/2 + 1,)] are scratch.
    The same steps as ``features.yin`` for one row: difference function, cumulative-mean
    normalisation, first dip under the threshold within an octave of ``expected_f0`` (else
    the minimum), its local minimum and a parabolic refinement.
    """
    w = x.size
    max_lag = w // 2
    lo = int(min(max(np.floor(sample_rate / (2.0 * expected_f0)), 2), max_lag - 2))
    hi = int(min(max(np.ceil(sample_rate / (0.5 * expected_f0)), 3), max_lag - 1))
    # Only lags up to hi + 1 are read below (the cumulative mean runs from lag 1 as in
    # the full-range computation, so these values are the same).
    top = min(hi + 1, max_lag)
    energy[0] = 0.0
    for i in range(top + max_lag):
        energy[i + 1] = energy[i] + x[i] * x[i]
    e_head = energy[max_lag]
    cmnd[0] = 1.0
    cum = 0.0
    for tau in range(1, top + 1):
        d = max(e_head + energy[tau + max_lag] - energy[tau] - 2.0 * cross[tau], 0.0)
        cum += d
        cmnd[tau] = d * tau / max(cum, AMIN)
    first = -1
    arg = lo
    for lag in range(lo, hi + 1):
        if cmnd[lag] < YIN_THRESHOLD:
            first = lag
            break
        if cmnd[lag] < cmnd[arg]:
            arg = lag
    if first < 0:
        first = arg if lo <= hi else 0
    best = first
    while best < hi and cmnd[best + 1] < cmnd[best]:
        best += 1
    best = min(max(best, 1), max_lag - 1)
    a = cmnd[best - 1]
    b = cmnd[best]
    c = cmnd[min(best + 1, max_lag)]
    denom = a - 2.0 * b + c
    shift = 0.5 * (a - c) / denom if abs(denom) > 1e-12 else 0.0
    period = best + min(max(shift, -1.0), 1.0)
    return sample_rate / period, min(max(b, 0.0), 1.0)
