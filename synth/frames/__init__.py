"""The ``frames`` engine: real violin frames chosen by a Viterbi search and overlap-added.

After the frame-concatenative violin synthesis of the seed paper: per target frame (f0,
energy, spectral centre of gravity derived from the actions, :mod:`synth.frames.targets`)
the N nearest database frames by Mahalanobis distance within the nearest k-means
centroids (:mod:`synth.frames.index`), a Viterbi search over them
(:mod:`synth.frames.viterbi_kernel`) and pitch-synchronous overlap-add with small pitch
corrections (:mod:`synth.frames.ola`). :class:`synth.frames.engine.FramesEngine` is
registered as engine ``"frames"``.
"""
