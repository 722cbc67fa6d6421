"""One path-following engine for every problem of hbm/ (forced responses, backbones).

:mod:`.problem` is what a problem offers the engine (solves, words, a row per
point), :mod:`.step` the step control's knobs, :mod:`.engine` the one
predictor-corrector loop, :mod:`.rows` the points recorded along the way.
"""
