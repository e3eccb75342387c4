"""Sound: synthesis engines behind one interface (the modal bowed string first).

Examples
--------
>>> from synth import BowControl, get_engine
>>> violin = get_engine("modal", "violin", seed=1)
>>> block = violin.process(256, {1: BowControl(bow_velocity=0.3, bow_force=0.6, beta=0.1)})
>>> block.audio.shape, block.audio.dtype
((256,), dtype('float32'))
"""

from synth.controls import Block, BowControl
from synth.engines import Engine, describe_engines, engine_names, get_engine, register_engine
from synth.instrument import Instrument
from synth.render import render_actions, render_with_diagnostics
from synth.strings import INSTRUMENT_NAMES, load_instrument

__all__ = ["INSTRUMENT_NAMES", "Block", "BowControl", "Engine", "Instrument", "describe_engines",
           "engine_names", "get_engine", "load_instrument", "register_engine", "render_actions",
           "render_with_diagnostics"]
