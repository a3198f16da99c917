"""Dead reckoning: constant course and speed from the start (a baseline)."""

from __future__ import annotations

import numpy as np

from ..physics.model import DynamicModel
from ..residual.features import ResidualConfig
from .forecast_setup import _check_flags, _check_row_stride, _forecast_setup, check_log_items
from .result import ForecastResult

__all__ = ["DeadReckoning"]


class DeadReckoning:
    """Constant course and speed from the start's 3-s average state (a baseline)."""

    name = "dead_reckoning"

    def __init__(self, vessel="gunnerus", *, start_average_s: float = 3.0):
        self.model = DynamicModel(vessel)
        self.config = ResidualConfig(start_average_s=start_average_s)

    def fit(self, logs=(), *, dp_only: bool = True, progress: bool = False, row_stride: int = 1):
        """Nothing to learn; returns self (the logs and the learners' options, when given,
        are checked as a fitting predictor checks them: :func:`~.forecast_setup.check_log_items`)."""
        # the learners' options, checked as they check them (a text 'no' is refused, not read as True)
        _check_flags(dp_only=dp_only, progress=progress)
        _check_row_stride(row_stride)
        check_log_items(logs)
        return self

    def forecast(self, log, start_times_s, horizon_s: float = 60.0, *, commands: str = "held") -> ForecastResult:
        """Constant-velocity tracks from every start time (``commands`` is checked, then unused)."""
        st = _forecast_setup(self.model, self.config, log, start_times_s, horizon_s, commands=commands)
        arrays, idx, H, eta0, nu0, lead = st.arrays, st.idx, st.H, st.eta0, st.nu0, st.lead_s
        c, s = np.cos(eta0[:, 2]), np.sin(eta0[:, 2])
        vn = c * nu0[:, 0] - s * nu0[:, 1]
        ve = s * nu0[:, 0] + c * nu0[:, 1]
        eta = np.empty((len(idx), H + 1, 3))
        eta[..., 0] = eta0[:, :1] + vn[:, None] * lead
        eta[..., 1] = eta0[:, 1:2] + ve[:, None] * lead
        eta[..., 2] = eta0[:, 2:3] + nu0[:, 2:3] * lead
        nu = np.broadcast_to(nu0[:, None, :], eta.shape).copy()
        return ForecastResult(arrays.time_s[idx], lead, eta, nu, flags=st.flags, notes=st.notes)
