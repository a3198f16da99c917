"""Adapters from published data sets into the project's log format.

* :mod:`~hybridship.datasets.esso_osaka`: the Esso Osaka free-running model tests
  (Osaka University).

The data never ship with the package: every loader takes the data folder (or file) as an
argument.
"""
