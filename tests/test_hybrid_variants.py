"""benchmarks/hybrid_variants.py: its options."""

import pytest

from conftest import load_benchmark


@pytest.mark.parametrize("bad", [["--members", "0"], ["--seed", "-1"]])
def test_an_ensemble_it_cannot_build_is_a_usage_error(bad, tmp_path, capsys):
    """--members below 1 or a negative --seed ended in EnsembleConfig's traceback after the
    logs were read and the physics scored; now a usage error (exit 2) naming the option."""
    hv = load_benchmark("hybrid_variants")
    with pytest.raises(SystemExit) as exc:
        hv.main([*bad, "--data", str(tmp_path), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"error: {bad[0]}: must be" in err, err
    assert not (tmp_path / "out").exists()


def test_the_docstring_names_every_file_the_run_writes(tmp_path, monkeypatch):
    """The docstring said --out writes hybrid_variants.md; the run also writes timing.csv (each
    variant's training time), which it did not name."""
    import re

    import numpy as np

    hv = load_benchmark("hybrid_variants")
    data = tmp_path / "logs"
    data.mkdir()
    (data / "a_seed1.csv.gz").write_bytes(b"")

    class Model:
        def __init__(self, *a, **kw):
            self.model = self

        vessel = None

        def fit(self, logs):
            return self

    monkeypatch.setattr(hv, "DynamicPredictor", Model)
    monkeypatch.setattr(hv, "HybridPredictor", Model)
    monkeypatch.setattr(hv, "as_log_arrays", lambda f, vessel: f)
    monkeypatch.setattr(hv.metrics, "drift_errors", lambda *a, **kw: np.ones((20, 4, 3)))
    out = tmp_path / "out"
    assert hv.main(["--data", str(data), "--members", "1", "--out", str(out)]) == 0
    written = sorted(p.name for p in out.iterdir())
    named = set(re.findall(r"``([\w.]+\.(?:md|csv))``", hv.__doc__))
    assert written == ["hybrid_variants.md", "timing.csv"]
    assert set(written) <= named, named
