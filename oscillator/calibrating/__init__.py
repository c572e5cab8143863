"""Calibration: the parameters of a model fitted to measured motion, with their uncertainty
(docs/calibration.md).

* :mod:`~oscillator.calibrating.measured`: measured steady responses, time series and event
  times, checked row by row;
* :mod:`~oscillator.calibrating.steady`: the model's responses at the measured points and their
  exact derivatives, each point's periodic orbit followed from one fit step to the next;
* :mod:`~oscillator.calibrating.series`: the model's trajectory at the measured times and its
  forward sensitivities through every switch;
* :mod:`~oscillator.calibrating.events`: the model's switch times matched to measured events,
  and their derivatives;
* :mod:`~oscillator.calibrating.uncertainty`: covariance, confidence intervals, correlations and
  the combinations of parameters the data cannot tell apart;
* :mod:`~oscillator.calibrating.fit`: :func:`calibrate`, least squares from one or several starts;
* :mod:`~oscillator.calibrating.store`: a calibration's resumable folder, each start kept as it ends.
"""
