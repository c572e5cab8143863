"""Robust design over an operating band (issue 39): :func:`~oscillator.designing.optimise.design`."""
