"""The orientation of y told by the physics: y written positive down (image rows) is named, and the diagnosis
of the flipped data is that of the data the right way up, not new physics."""
import shutil

import numpy as np

from validation.diagnosis import DiagnoseConfig, diagnose_dataset
from validation.diagnosis.calibrate.orientation import FAR_BETTER, judge_inverted


# the velocity coupling's trajectory test (on by default; trajectory_test=False below) is not what
# this module checks: it is checked in test_velocity_output_error.py and, end to end, in
# test_pipeline_twin.py, and costs 10-15 CPU-s per diagnosis

def _write_upside_down(up, down):
    down.mkdir()
    shutil.copy(up / "meta.json", down / "meta.json")
    for f in sorted(up.glob("*.csv")):
        out, header = [], None
        for line in f.read_text().splitlines():
            if line.startswith("#") or header is None:
                header = header if line.startswith("#") else line.split(",")
                out.append(line)
                continue
            cells = line.split(",")
            i = header.index("y")
            if cells[i] not in ("", "nan"):
                cells[i] = repr(-float(cells[i]))
            out.append(",".join(cells))
        (down / f.name).write_text("\n".join(out) + "\n")


def test_y_positive_down_is_named_and_not_reported_as_new_physics(tmp_path):
    """5 runs of 1.5 s with pair scattering (kappa 15,000 1/s^2), written with y positive down; alpha 0.05 so that
    5 runs can identify an effect (smallest sign-flip p 2^-5)."""
    from validation.blind.twin_like import TwinLikeConfig, write_twin_like_dataset
    from validation.report.sections.gap_diagnosis import diagnosis_section

    up, down = tmp_path / "up", tmp_path / "down"
    truth = write_twin_like_dataset(up, TwinLikeConfig(runs=5, duration=1.5, seed=3, pressure_error=0.05,
                                                       effects={"pair_scattering": {"kappa": 15000.0}}))
    _write_upside_down(up, down)
    diag = diagnose_dataset(down, DiagnoseConfig(long_time=False, alpha=0.05, trajectory_test=False), progress=False)
    (w,) = diag.data_warnings
    assert w["code"] == "y_inverted" and "y -> -y" in w["message"] and "\n" not in w["message"]
    # the trap's asymmetry: the vertical equation of the recorded (inverted) data keeps a gap far above the flipped
    assert w["vertical_gap_flipped"] <= FAR_BETTER * w["vertical_gap"]
    # diagnosed with -y: the effect built in is named, with its parameter, and nothing is left to discover
    assert diag.identified == ("pair_scattering",)
    kappa = diag.effects[0].params["kappa"]
    # 5 runs of 1.5 s with 1-um / 0.005 tracking noise: kappa within 10 % (the blind study's errors at this size
    # are a few per cent)
    np.testing.assert_allclose(kappa, truth["effects"]["pair_scattering"]["kappa"], rtol=0.10)
    assert diag.remaining_gap["discovered_terms"] == {"yddot": [], "thetaddot": []}
    # the report says so first
    assert diagnosis_section(diag, []).reading.startswith("Data warning: y evidently points down")


def test_the_judgement_is_one_sided():
    """The same gaps the other way round (the data the right way up) are not flagged, nor gaps the noise makes."""
    g, gf = np.array([0.03, 0.02, 0.04]), np.array([1e-4, 2e-4, 5e-5])
    assert judge_inverted(g, gf) and not judge_inverted(gf, g)
    assert not judge_inverted(1e-3 * g, 1e-3 * gf)  # below MIN_VERTICAL_GAP: noise, not orientation
    assert not judge_inverted(g, np.r_[gf[:2], 0.05])  # one run fits worse flipped: not evident
