"""Analyses built on :func:`oscillator.simulate`: parameter sweeps (Sec. 7), locating where a sweep's
summary changes, and the comparison with the article's reported times."""
