"""Sound: synthesis engines behind one interface (the modal bowed string first).

Names load on first use (PEP 562, :mod:`data_schemas.lazy`): ``import synth`` and the engine
registry (:func:`engine_names`, :func:`describe_engines`) import neither numpy nor numba.

Examples
--------
>>> from synth import BowControl, get_engine
>>> violin = get_engine("modal", "violin", seed=1)
>>> block = violin.process(256, {1: BowControl(bow_velocity=0.3, bow_force=0.6, beta=0.1)})
>>> block.audio.shape, block.audio.dtype
((256,), dtype('float32'))
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from data_schemas.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - where each name lives (read by lazy_exports)
    from synth.controls import Block, BowControl
    from synth.engines import (
        DEFAULT_ENGINE,
        Engine,
        describe_engines,
        engine_names,
        get_engine,
        register_engine,
    )
    from synth.instrument import Instrument
    from synth.render import render_actions, render_with_diagnostics
    from synth.strings import INSTRUMENT_NAMES, load_instrument

__all__ = ["DEFAULT_ENGINE", "INSTRUMENT_NAMES", "Block", "BowControl", "Engine", "Instrument",
           "describe_engines", "engine_names", "get_engine", "load_instrument",
           "register_engine", "render_actions", "render_with_diagnostics"]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
