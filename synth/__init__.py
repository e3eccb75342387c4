"""Sound: string constants, the modal bowed-string kernel, body, and the instrument."""

from synth.instrument import BowControl, Instrument
from synth.render import render_actions, render_with_diagnostics
from synth.strings import INSTRUMENT_NAMES, load_instrument

__all__ = ["INSTRUMENT_NAMES", "BowControl", "Instrument", "load_instrument", "render_actions",
           "render_with_diagnostics"]
