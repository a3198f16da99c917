"""hybridship: ship motion forecasting with a 3-DOF Fossen model and neural residual ensembles."""

__version__ = "0.1.0"
