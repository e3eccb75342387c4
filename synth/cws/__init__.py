"""The ``cws`` engine: cluster-weighted sampling of recorded violin audio (Schoner et al. 2000).

Modules: :mod:`~synth.cws.cwm` (the cluster-weighted model and its EM fit),
:mod:`~synth.cws.resample_kernel` (eq. 5's sinc resampler), :mod:`~synth.cws.joins`
(eqs. 6-8: volume scaling, cross-correlation alignment, sin^2 cross-fades),
:mod:`~synth.cws.training` (features of an audio-frame database and the trained model),
:mod:`~synth.cws.notes` (notes of an actions table), :mod:`~synth.cws.synthesis` (attack
samples + harmonic sustain) and :mod:`~synth.cws.engine` (the engine).
"""
