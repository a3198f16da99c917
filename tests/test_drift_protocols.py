"""benchmarks/drift_protocols.py: its decisions file on hand-made ``training_info``."""

from types import SimpleNamespace

import numpy as np

from conftest import load_benchmark
from hybridship.residual.drift_hull import MUNK_MULTIPLES, choose_coefficient


def _fit(drift_hull=None, thrust_error_prior=None, dp_only=False, uses_drift_hull=True, wave_yaw_load=None):
    """A fitted predictor as :func:`decision` reads it."""
    info = {"calibration": {"dp_only": dp_only}}
    if drift_hull is not None:
        info["drift_hull"] = drift_hull
    if thrust_error_prior is not None:
        info["thrust_error_prior"] = thrust_error_prior
    if wave_yaw_load is not None:
        info["wave_yaw_load"] = wave_yaw_load
    return SimpleNamespace(training_info=info, uses_drift_hull=uses_drift_hull,
                           turns_yaw_load=bool(wave_yaw_load and wave_yaw_load["turned"]))


def test_the_decisions_file_has_a_row_per_fit_and_counts_what_was_kept(tmp_path):
    dp = load_benchmark("drift_protocols")
    # the hull's yaw moment as fit records it: 0 x Munk worst everywhere, so a non-zero one is kept
    obj = np.tile(np.abs(MUNK_MULTIPLES - 0.65)[:, None], (1, 5)) + np.linspace(0.0, 0.01, 5)
    kept_hull = {**choose_coefficient(obj, 0.005).as_dict(), "horizon_s": 60.0, "start_every_s": 10.0}
    assert kept_hull["adopted"]
    checked = {"learned_mean": [0.48, -0.09, -0.14], "learned_std": [0.1, 0.1, 0.2], "n_failures": 5,
               "horizon_s": 60.0, "kept": False, "position_error_m": [1.433, 1.4334],
               "heading_error_deg": [1.96, 2.0], "position_p_value": 0.5, "heading_p_value": 0.7}
    # a hull's yaw moment chosen on too few failures to pass the left-out check: chosen, not kept
    obj3 = np.tile(np.abs(MUNK_MULTIPLES - 0.65)[:, None], (1, 3)) + np.linspace(0.0, 0.01, 3)
    unkept_hull = {**choose_coefficient(obj3, 0.005).as_dict(), "horizon_s": 60.0, "start_every_s": 10.0}
    assert not unkept_hull["adopted"]
    few = {"learned_mean": [0.1, 0.0, 0.0], "learned_std": [0.1, 0.1, 0.2], "n_failures": 2, "horizon_s": 60.0,
           "kept": False}
    # the yaw load turned with the waves as fit records its choice ("auto", the default)
    turned = {"n_failures": 5, "held_deg": 1.54, "turned_deg": 1.42, "n_gains": 5, "p_value": 0.03125,
              "turned": True, "horizon_s": 60.0, "start_every_s": 10.0}
    decisions = [dp.decision("a", "paper", "all", _fit(dp_only=True, uses_drift_hull=False)),
                 dp.decision("a", "fleet_default", "log0", _fit(kept_hull, dp_only=True, wave_yaw_load=turned)),
                 dp.decision("a", "fleet", "log0", _fit(kept_hull, checked)),
                 dp.decision("b", "fleet", "s0", _fit(None, few, wave_yaw_load={"n_failures": 2, "turned": False})),
                 dp.decision("b", "sim_pretrain", "all", _fit(unkept_hull, {**few, "kept": True}))]
    text = dp.decisions_markdown(decisions)
    lines = text.splitlines()
    rows = [x for x in lines if x.startswith("| ") and not x.startswith("| ---")]
    assert len(rows) == 1 + len(decisions)                 # header, then one row per fit
    assert rows[1].startswith("| a | paper | all | off (`drift_hull=False`) | not learned (DP parts only) |")
    assert rows[1].endswith("| held (`drift_hull=False`: nothing learned from failures) |")
    assert rows[2].endswith("| turned with the waves: heading 1.54 deg held, 1.42 turned on 5 failures, 5 gain, "
                            "signed-rank p = 0.0312 |")
    assert rows[4].endswith("| held (2 failures, fewer than 5) |") and rows[3].endswith("| held |")
    assert "0.65 x Munk on 5 failures, kept: heading " in rows[2]
    assert "with it chosen on the others (left out), 5 of 5 better, signed-rank p = 0.0312" in rows[2]
    assert "not kept: learned (+0.48, -0.09, -0.14) with 5 failures" in rows[3]
    assert "position 1.433 m against 1.433 m, heading 2.00 deg against 1.96 deg" in rows[3]
    assert "not chosen (fewer than 5 failures)" in rows[4] and "fewer than the 5 the check needs" in rows[4]
    assert "0.65 x Munk on 3 failures, not kept: heading " in rows[5]
    assert lines[-2:] == [
        "* a: thrust error kept in 0 of 1 fit that learned it; hull's yaw moment in a drift kept in 2 of 2 "
        "fits that chose one; yaw load turned with the waves in 1 of 3 fits.",
        "* b: thrust error kept in 1 of 2 fits that learned it; hull's yaw moment in a drift kept in 0 of 1 "
        "fit that chose one; yaw load turned with the waves in 0 of 2 fits."]     # counts the kept, not the chosen
    assert text.endswith(".\n")


def test_the_dp_part_cuts_every_per_row_array_before_the_first_shutdown():
    """``sim_pretrain`` trains on the own logs' DP parts: every per-row array (``commands_logged``
    too, which the nets' rows read) ends at the first row with the DP off."""
    from hybridship.predictors import HybridPredictor, as_log_arrays
    from hybridship.sim.scenario import embedded_scenarios

    dp = load_benchmark("drift_protocols")
    a = as_log_arrays(embedded_scenarios(1, 0)[0].log, HybridPredictor("gunnerus").model.vessel)
    end = int(np.flatnonzero(a.dp_active == 0)[0])
    b = dp._dp_part(a)
    assert len(b) == end and b.dp_active.all()
    for name in ("time_s", "eta", "rpm", "dp_active", "segment_id", "wind_logged", "commands_logged"):
        np.testing.assert_array_equal(getattr(b, name), getattr(a, name)[:end])


def test_a_hull_chosen_on_one_failure_and_a_fit_without_a_thrust_stop_say_so():
    """With one failure there is nothing to leave out, and a fit that read the drifts but
    found no thrust stop learned no thrust error: both cells say which, not the DP-only text."""
    dp = load_benchmark("drift_protocols")
    obj = np.abs(MUNK_MULTIPLES - 0.65)[:, None]           # one failure, best at 0.65 x Munk
    hull = {**choose_coefficient(obj, 0.005).as_dict(), "horizon_s": 60.0, "start_every_s": 10.0}
    row = [x for x in dp.decisions_markdown([dp.decision("c", "fleet", "s1", _fit(hull))]).splitlines()
           if x.startswith("| c ")]
    # 0.65 rad of heading error without the moment, none with it
    assert row == [f"| c | fleet | s1 | 0.65 x Munk on 1 failures, not kept: heading {np.degrees(0.65):.2f} deg "
                   "without it, 0.00 with it, no left-out check | not learned (no thrust stop read) | held |"]


def test_counts_and_seeds_it_cannot_use_are_usage_errors(tmp_path, capsys):
    """--sim-scenarios outside 1-20, --embedded outside 0-20, --members below 1 or a negative
    --seed stop with a usage error (exit 2) naming the option, before any work (they ended in
    a library traceback)."""
    import pytest

    protocols = load_benchmark("drift_protocols")
    for bad in (["--sim-scenarios", "0"], ["--sim-scenarios", "21"], ["--embedded", "21"], ["--embedded", "-1"],
                ["--members", "0"], ["--seed", "-1"]):
        with pytest.raises(SystemExit) as exc:
            protocols.main([*bad, "--out", str(tmp_path)])
        assert exc.value.code == 2
        assert bad[0] in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_a_data_set_too_small_to_leave_one_log_out_is_a_usage_error(tmp_path, capsys, monkeypatch):
    """--embedded 1 fitted its fold on no log, and --embedded 0 without truthsim-dev scored
    nothing: each ended in a library traceback after minutes of work."""
    import pytest

    protocols = load_benchmark("drift_protocols")
    monkeypatch.setattr(protocols, "TRUTHSIM", tmp_path / "absent")
    for bad, expected in ((["--embedded", "1"], "expected 0 or 2-20 "), (["--embedded", "0"], "expected 2-20, as ")):
        with pytest.raises(SystemExit) as exc:
            protocols.main([*bad, "--out", str(tmp_path / "out")])
        assert exc.value.code == 2
        assert f"--embedded: {expected}" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
