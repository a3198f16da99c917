"""benchmarks/hull_yaw_residual.py: its options."""

import pytest

from conftest import load_benchmark


@pytest.mark.parametrize("cutoff", ["0", "-0.1", "nan", "0.5"])
def test_a_cutoff_the_low_pass_cannot_take_is_a_usage_error(cutoff, tmp_path, capsys):
    """--cutoff-hz at or below 0, NaN, or at or above half the logs' sample rate (0.5 Hz for a
    1-Hz log) failed in scipy's traceback ('Digital filter critical frequencies must be
    0 < Wn < fs/2'), naming no option; it is now a usage error (exit 2) naming --cutoff-hz."""
    import numpy as np
    import pandas as pd

    hy = load_benchmark("hull_yaw_residual")
    data = tmp_path / "logs"
    data.mkdir()
    pd.DataFrame({"time_s": np.arange(100.0), "dp_active": 1}).to_csv(data / "a.csv", index=False)
    with pytest.raises(SystemExit) as exc:
        hy.main(["--data", str(data), "--out", str(tmp_path / "out"), "--cutoff-hz", cutoff])
    assert exc.value.code == 2
    assert "error: --cutoff-hz: expected a frequency" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
