"""Evaluation: forecast errors and the benchmarks that compare forecasters on the same starts.

* :mod:`~hybridship.evaluation.metrics`: forecasts after a shutdown and their errors at
  15/30/45/60 s (Skulstad et al. 2022, Table 2);
* :mod:`~hybridship.evaluation.drift`: the drift benchmark (Tables 2 and 3, coverage,
  figures) on any folder of logs (``hybridship benchmark drift``);
* :mod:`~hybridship.evaluation.manoeuvre`: the manoeuvring benchmark on free-running runs
  such as Esso Osaka (``hybridship benchmark manoeuvre``).

Nothing is imported here, so that a forecaster can use :mod:`~hybridship.evaluation.metrics`
without loading the benchmarks (which import the forecasters).
"""
