"""What goes into an engine and what comes out: per-string bowing controls and audio blocks."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from synth.diagnostics import ContactDiagnostics

#: Output samples per coefficient update of beta and finger (1.45 ms at 44.1 kHz).
SUB_BLOCK = 64
#: A pluck pulls the string this far (m) at this speed (m/s), then lets go: 1 mm in 10 ms.
#: Artifastring pulls 5 mm; measured here that made a mezzo-forte pluck peak 7x above a
#: mezzo-forte bowed note (1.0 against 0.14 of full scale on the violin D string); 1 mm
#: puts plucks at bowed levels.
PLUCK_DISPLACEMENT = 0.001
PLUCK_SPEED = 0.1

@dataclass(frozen=True)
class BowControl:
    """Bowing of one string at the end of a block.

    Attributes
    ----------
    bow_velocity : float, m/s (+ = down-bow)
    bow_force : float, N
    beta : float
        Bow-bridge distance / effective string length.
    finger_ratio : float
        Fraction of the string length removed by the finger (0 = open).
    finger_touch : bool
        The finger only touches the string at ``finger_ratio`` (natural harmonics).
    """

    bow_velocity: float
    bow_force: float
    beta: float
    finger_ratio: float = 0.0
    finger_touch: bool = False


@dataclass
class StringInput:
    """Controls of one string over a run at the internal rate.

    Attributes
    ----------
    bow_velocity, bow_force : np.ndarray [shape=(n_internal,)], m/s and N
    contact : np.ndarray [shape=(n_internal,)], int8
        Per sample :data:`synth.modal_kernel.CONTACT_LIFTED`, ``CONTACT_BOW`` or
        ``CONTACT_GRIP``.
    beta, finger_ratio : np.ndarray [shape=(n_sub_blocks,)]
        One value per :data:`SUB_BLOCK` output samples (a single value when
        ``steady_contact``).
    pluck_offsets : sequence of int
        Internal-sample offsets in this run where plucks start.
    pluck_pulls : sequence of float, m
        How far each pluck pulls the string before letting go (default
        :data:`PLUCK_DISPLACEMENT`).
    steady_contact : bool
        beta, finger_ratio and finger_touch are the same over the whole run (one kernel
        call).
    finger_touch : np.ndarray [shape=(n_sub_blocks,)], bool, optional
        Per sub-block, the finger only touches the string (None: it stops it throughout).
    touch_ratio : np.ndarray [shape=(n_sub_blocks,)], optional
        Per sub-block, a second, touching finger's distance from the nut / string length
        while ``finger_ratio`` stops the string (NaN or None: no second finger).
    """

    bow_velocity: np.ndarray
    bow_force: np.ndarray
    contact: np.ndarray
    beta: np.ndarray
    finger_ratio: np.ndarray
    pluck_offsets: tuple[int, ...] = ()
    pluck_pulls: tuple[float, ...] = ()
    steady_contact: bool = False
    finger_touch: np.ndarray | None = None
    touch_ratio: np.ndarray | None = None


@dataclass
class Block:
    """Output of :meth:`Instrument.process`.

    Attributes
    ----------
    audio : np.ndarray [shape=(n_samples,)], float32
    bridge_force : np.ndarray [shape=(n_samples,)], N
        Summed bridge force after decimation, before the body.
    diagnostics : dict of int to ContactDiagnostics
        Per string that has been excited, over the whole block.
    hop_diagnostics : dict of int to list of ContactDiagnostics
        The same per hop, when the block was run with a hop size (else empty).
    """

    audio: np.ndarray
    bridge_force: np.ndarray
    diagnostics: dict[int, ContactDiagnostics]
    hop_diagnostics: dict[int, list[ContactDiagnostics]] = field(default_factory=dict)
