"""What labs write (docs/formats.md): each variant a small fixture.

Files that are read (unit labels, separators, decimal comma, BOM and CRLF, a frame column, omitted rows of lost
frames) must give the same run as the plain SI file; conventions that are wrong (milliseconds, micrometres,
millimetres, an absolute height, pure noise, degrees) are refused by name with what to do, with or without
meta.json, and a command refusing a data set exits 2 with one line and writes nothing.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from cubedimer.dataset import DatasetError, load_dataset, load_run

FPS, F_Y, F_THETA = 2000.0, 21.8, 9.0
N_FRAMES = 3000  # 1.5 s: 33 vertical periods, well above the 5 the loader asks for


def _run(seed: int = 0):
    """A damped 21.8-Hz vertical and 9-Hz hinge oscillation with 1-um tracking noise (SI units)."""
    rng = np.random.default_rng(seed)
    t = np.arange(N_FRAMES) / FPS
    y = (1e-4 * np.exp(-0.3 * t) * np.cos(2 * np.pi * F_Y * t + rng.uniform(0, 6))
         + 1e-6 * rng.standard_normal(t.size))
    th = 0.2 * np.exp(-0.5 * t) * np.cos(2 * np.pi * F_THETA * t + rng.uniform(0, 6))
    return t, y, th


def _write(path, header, rows, sep=",", decimal=".", newline="\n", bom=False):
    def cell(v):
        if isinstance(v, str):
            return v
        text = "" if not np.isfinite(v) else repr(float(v))
        return text.replace(".", decimal)

    lines = [sep.join(header)] + [sep.join(cell(v) for v in row) for row in rows]
    data = newline.join(lines) + newline
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + data.encode())
    return path


def _dataset(tmp_path, n=4, transform=None, header=("t", "y", "theta"), meta=None, **kw):
    d = tmp_path / "data"
    d.mkdir()
    for i in range(n):
        t, y, th = _run(i)
        if transform:
            t, y, th = transform(t, y, th)
        _write(d / f"run{i + 1:02d}.csv", header, zip(t, y, th), **kw)
    if meta is not None:
        (d / "meta.json").write_text(json.dumps(meta))
    return d


# ------------------------------------------------------------------------------------------------- read
@pytest.mark.parametrize("header, scale", [
    (("t [s]", "y [m]", "theta [-]"), (1.0, 1.0)),
    (("t (s)", "y (m)", "theta"), (1.0, 1.0)),
    (("t [ms]", "y [um]", "theta [-]"), (1e3, 1e6)),    # contradicting labels, unambiguous: converted
    (("T [MS]", "Y [mm]", "Theta"), (1e3, 1e3)),
    (("t [\u00b5s]", "y (\u00b5m)", "theta [1]"), (1e6, 1e6)),
])
def test_unit_labels_are_read_and_converted(tmp_path, header, scale):
    t, y, th = _run()
    p = _write(tmp_path / "r.csv", header, zip(t * scale[0], y * scale[1], th))
    run = load_run(p)
    # the labels' factors are exact powers of ten: the SI file's numbers to the last bits of repr()
    np.testing.assert_allclose(run.t, t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(run.y, y, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(run.theta, th, rtol=0, atol=0)


@pytest.mark.parametrize("sep, decimal", [(";", "."), ("\t", "."), (";", ","), ("\t", ",")])
@pytest.mark.parametrize("newline, bom", [("\n", False), ("\r\n", True)])
def test_separators_decimal_comma_bom_and_crlf(tmp_path, sep, decimal, newline, bom):
    t, y, th = _run()
    p = _write(tmp_path / "r.csv", ("t", "y", "theta"), zip(t, y, th), sep=sep, decimal=decimal, newline=newline,
               bom=bom)
    run = load_run(p)
    # repr() round-trips floats exactly, and the decimal comma is a character swap
    assert np.array_equal(run.t, t) and np.array_equal(run.y, y) and np.array_equal(run.theta, th)


def test_frame_column_with_frame_rate_in_meta(tmp_path):
    d = tmp_path / "data"
    d.mkdir()
    for i in range(3):
        t, y, th = _run(i)
        frames = np.arange(t.size) + 17  # the recording's own frame numbers
        _write(d / f"run{i}.csv", ("frame", "y", "theta"), ((str(f), a, b) for f, a, b in zip(frames, y, th)))
    (d / "meta.json").write_text(json.dumps({"frame_rate_hz": FPS}))
    ds = load_dataset(d)
    assert len(ds.runs) == 3 and not ds.skipped
    # t = frame / frame rate: steps of exactly 1/2000 s
    np.testing.assert_allclose(np.diff(ds.runs[0].t), 1.0 / FPS, rtol=1e-12)
    np.testing.assert_allclose(ds.runs[0].t[0], 17 / FPS, rtol=1e-12)


def test_frame_column_without_frame_rate_says_what_is_missing(tmp_path):
    t, y, th = _run()
    p = _write(tmp_path / "r.csv", ("frame", "y", "theta"), ((str(i), a, b) for i, (a, b) in enumerate(zip(y, th))))
    with pytest.raises(DatasetError, match="frame_rate_hz in meta.json"):
        load_run(p)


def test_omitted_rows_of_lost_frames_are_filled_as_missing(tmp_path):
    t, y, th = _run()
    keep = np.ones(t.size, bool)
    keep[[400, 401, 402, 1500, 2222]] = False  # a tracker leaves out the frames it lost
    p = _write(tmp_path / "r.csv", ("t", "y", "theta"), zip(t[keep], y[keep], th[keep]))
    run = load_run(p)
    assert run.t.size == t.size and run.n_filled == 5
    np.testing.assert_allclose(run.t, t, rtol=0, atol=1e-12)
    # PCHIP across a 3-frame hole (span 2 ms) of a 21.8-Hz, 100-um oscillation: error <= A (omega D)^2 / 8 = 9 um
    # (plus the 1-um noise of the neighbours)
    np.testing.assert_allclose(run.y[400:403], y[400:403], atol=1e-4 * (2 * np.pi * F_Y * 0.002) ** 2 / 8 + 4e-6)


def test_a_step_that_is_not_a_whole_number_of_frames_names_the_remedy(tmp_path):
    t, y, th = _run()
    t = t.copy()
    t[1000:] += 0.4 / FPS
    p = _write(tmp_path / "r.csv", ("t", "y", "theta"), zip(t, y, th))
    with pytest.raises(DatasetError) as err:
        load_run(p)
    msg = str(err.value)
    assert "not uniformly sampled" in msg and "empty y and theta" in msg and "\n" not in msg


# -------------------------------------------------------------------------------------------- refused
def test_lab_column_names_report_every_missing_column_and_the_accepted_names(tmp_path):
    t, y, th = _run()
    p = _write(tmp_path / "r.csv", ("time", "y", "angle"), zip(t, y, th))
    with pytest.raises(DatasetError) as err:
        load_run(p)
    msg = str(err.value)
    assert "missing columns 't', 'theta'" in msg
    assert "accepted names: t [s], y [m], theta [-]" in msg and "'time' -> 't'" in msg and "'angle' -> 'theta'" in msg


@pytest.mark.parametrize("label, hint", [("deg", "divide it by 180"), ("rad", "by pi"), ("\u00b0", "by 180")])
def test_theta_in_degrees_is_refused_with_the_conversion(tmp_path, label, hint):
    t, y, th = _run()
    p = _write(tmp_path / "r.csv", ("t", "y", f"theta [{label}]"), zip(t, y, 180 * th))
    with pytest.raises(DatasetError, match=hint):
        load_run(p)


def test_unlabelled_degrees_name_the_conversion(tmp_path):
    t, y, th = _run()
    p = _write(tmp_path / "r.csv", ("t", "y", "theta"), zip(t, y, 180 * th))
    with pytest.raises(DatasetError, match="outside .* divide by 180"):
        load_run(p)


@pytest.mark.parametrize("header", [("t", "y [px]", "theta"), ("t [fortnight]", "y", "theta")])
def test_ambiguous_or_unknown_labels_are_refused(tmp_path, header):
    t, y, th = _run()
    p = _write(tmp_path / "r.csv", header, zip(t, y, th))
    with pytest.raises(DatasetError, match="pixel size|unknown unit label"):
        load_run(p)


#: The convention mistakes of the first hour, each with the start of its message.
MISTAKES = {
    "milliseconds": (lambda t, y, th: (1e3 * t, y, th), "t looks like milliseconds"),
    "microseconds": (lambda t, y, th: (1e6 * t, y, th), "t looks like microseconds"),
    "micrometres": (lambda t, y, th: (t, 1e6 * y, th), "y looks like micrometres"),
    "millimetres": (lambda t, y, th: (t, 1e3 * y, th), "y looks like millimetres"),
    "absolute height": (lambda t, y, th: (t, 12.3e-3 + y, th), "y looks like an absolute height"),
    "pure noise": (lambda t, y, th: (t, 1e-6 * np.random.default_rng(9).standard_normal(t.size), th),
                   "pure noise"),
}


@pytest.mark.parametrize("meta", [None, {"side_length_m": 5e-4}], ids=["no-meta", "meta"])
@pytest.mark.parametrize("mistake", list(MISTAKES))
def test_convention_mistakes_refuse_the_set_with_or_without_meta(tmp_path, mistake, meta):
    transform, cause = MISTAKES[mistake]
    d = _dataset(tmp_path, transform=transform, meta=meta)
    with pytest.raises(DatasetError) as err:
        load_dataset(d)
    msg = str(err.value)
    assert "no usable runs: every file fails the same check" in msg and cause in msg and "\n" not in msg
    assert "docs/conventions.md" in msg or mistake == "pure noise"


def test_one_file_in_milliseconds_among_good_ones_is_skipped_by_name(tmp_path):
    d = _dataset(tmp_path, n=2)
    t, y, th = _run(7)
    _write(d / "run03.csv", ("t", "y", "theta"), zip(1e3 * t, y, th))
    ds = load_dataset(d)
    assert [r.name for r in ds.runs] == ["run01.csv", "run02.csv"]
    assert ds.skipped[0].file == "run03.csv" and ds.skipped[0].reason.startswith("t looks like milliseconds")


def test_unknown_meta_keys_are_named_with_the_known_ones(tmp_path, caplog):
    d = _dataset(tmp_path, n=1, meta={"side": 0.0005, "pressure": 3000, "source": "lab notebook 4"})
    with caplog.at_level("WARNING", logger="cubedimer.meta"):
        load_dataset(d)
    (rec,) = [r for r in caplog.records if r.name == "cubedimer.meta"]
    msg = rec.getMessage()
    assert "'side', 'pressure'" in msg and "side_length_m" in msg and "pressure_amplitude_pa" in msg
    assert "source" not in msg.split("ignored")[0]  # a free-text key is not unknown


TRACKING_BLOCK = {"noise_y_m": 1.2e-7, "noise_theta": 5e-4, "fraction_measured": 0.998, "frames": 4000,
                  "pixel_size_m": 1e-5, "side_length_m_measured": 5.02e-4, "runs": [], "skipped": [], "method": "m"}


def test_the_tracking_block_is_a_known_key_read_without_a_warning(tmp_path, caplog):
    d = _dataset(tmp_path, n=1, meta={"tracking": TRACKING_BLOCK})
    with caplog.at_level("WARNING", logger="cubedimer.meta"):
        ds = load_dataset(d)
    assert not [r for r in caplog.records if r.name == "cubedimer.meta"]
    assert ds.meta["tracking"] == TRACKING_BLOCK


@pytest.mark.parametrize("block,named", [
    ([1, 2], "'tracking' must be a JSON object"),
    (dict(TRACKING_BLOCK, noise_y_m=-1e-7), "tracking.noise_y_m = -1e-07 must be a number in [0, 0.01]"),
    (dict(TRACKING_BLOCK, fraction_measured=1.5), "tracking.fraction_measured = 1.5"),
    (dict(TRACKING_BLOCK, noise_theta="small"), "tracking.noise_theta = 'small'"),
])
def test_a_bad_tracking_block_is_one_line_naming_the_key(tmp_path, block, named):
    d = _dataset(tmp_path, n=1, meta={"tracking": block})
    with pytest.raises(DatasetError) as err:
        load_dataset(d)
    assert named in str(err.value) and "meta.json" in str(err.value) and "\n" not in str(err.value)


# ------------------------------------------------------------------------------------- the commands
def _one_line_refusal(capsys, main, argv, out):
    rc = main(argv)
    err = capsys.readouterr().err.strip()
    assert rc == 2, err
    assert err.startswith("error: ") and "\n" not in err, err
    assert not out.exists()
    return err


@pytest.mark.parametrize("mistake", ["milliseconds", "micrometres", "absolute height", "pure noise"])
def test_fit_refuses_a_set_in_the_wrong_convention(tmp_path, capsys, mistake):
    from fitting.cli import main

    transform, cause = MISTAKES[mistake]
    d = _dataset(tmp_path, transform=transform)
    err = _one_line_refusal(capsys, main, ["fit", str(d), "--out", str(tmp_path / "fit"), "--workers", "1"],
                            tmp_path / "fit")
    assert cause in err


@pytest.mark.parametrize("mistake", ["milliseconds", "micrometres"])
def test_diagnose_refuses_a_set_in_the_wrong_convention(tmp_path, capsys, mistake):
    from validation.cli import main

    transform, cause = MISTAKES[mistake]
    d = _dataset(tmp_path, transform=transform)
    err = _one_line_refusal(capsys, main, ["diagnose", str(d), "--out", str(tmp_path / "diag"), "--quiet"],
                            tmp_path / "diag")
    assert cause in err


def test_fit_refuses_lab_column_names_in_one_line(tmp_path, capsys):
    from fitting.cli import main

    d = _dataset(tmp_path, header=("time", "y", "angle"))
    err = _one_line_refusal(capsys, main, ["fit", str(d), "--out", str(tmp_path / "fit"), "--workers", "1"],
                            tmp_path / "fit")
    assert "missing columns 't', 'theta'" in err
